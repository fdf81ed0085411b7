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

use tiny_skia::{
    FillRule, LineCap, LineJoin, Mask, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform,
};

use super::colour::{self, Colour};
use super::draw::{nice, stroke_line};
use super::text::{Align, draw_text, draw_text_vertical, text_width, vertical_metrics};
use super::{Quality, RenderError, check_size, export};

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

/// One tick of an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Tick {
    /// Position in data units.
    pub value: f64,
    /// Label; empty for a minor tick.
    pub label: String,
}

/// An axis: its ends in data units, its scale and its ticks (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Value at the start (left or bottom).
    pub lo: f64,
    /// Value at the end (right or top).
    pub hi: f64,
    /// Linear or log.
    pub scale: Scale,
    /// Ticks from `lo` to `hi`.
    pub ticks: Vec<Tick>,
}

impl Axis {
    /// Nice linear ticks over `[a, b]` with about `n` ticks (module docs). An empty or
    /// degenerate range is widened.
    #[must_use]
    pub fn linear(a: f64, b: f64, n: usize) -> Axis {
        let (mut a, mut b) = if a <= b { (a, b) } else { (b, a) };
        if !(a.is_finite() && b.is_finite()) {
            (a, b) = (0.0, 1.0);
        }
        if b - a <= f64::EPSILON * a.abs().max(b.abs()).max(1e-300) {
            let w = if a == 0.0 { 1.0 } else { 0.1 * a.abs() };
            (a, b) = (a - w, b + w);
        }
        let range = nice(b - a, false);
        let d = nice(range / (n.max(2) - 1) as f64, true);
        let lo = (a / d).floor() * d;
        let hi = (b / d).ceil() * d;
        let decimals = (-d.log10().floor()).max(0.0) as usize;
        let scientific = lo.abs().max(hi.abs()) >= 1e6 || d < 1e-4;
        let count = ((hi - lo) / d).round() as i64;
        let ticks = (0..=count)
            .map(|k| {
                let v = lo + k as f64 * d;
                // Snap values that should be 0 (from lo + k d rounding).
                let v = if v.abs() < 1e-9 * d { 0.0 } else { v };
                Tick {
                    value: v,
                    label: if scientific {
                        scientific_label(v, d)
                    } else {
                        format!("{v:.decimals$}")
                    },
                }
            })
            .collect();
        Axis {
            lo,
            hi,
            scale: Scale::Linear,
            ticks,
        }
    }

    /// Decade ticks over `[a, b]`, `0 < a ≤ b` (module docs). Non-positive input gives 1 to 10.
    #[must_use]
    pub fn log(a: f64, b: f64) -> Axis {
        let (a, b) = if a > 0.0 && b >= a && b.is_finite() {
            (a, b)
        } else {
            (1.0, 10.0)
        };
        let k0 = a.log10().floor() as i32;
        let mut k1 = b.log10().ceil() as i32;
        if k1 <= k0 {
            k1 = k0 + 1;
        }
        let decades = (k1 - k0) as usize;
        let every = decades.div_ceil(8).max(1);
        let mut ticks = Vec::new();
        for k in k0..=k1 {
            let labelled = ((k - k0) as usize).is_multiple_of(every);
            ticks.push(Tick {
                value: 10f64.powi(k),
                label: if labelled {
                    power_of_ten(k)
                } else {
                    String::new()
                },
            });
            if decades <= 6 && k < k1 {
                for m in 2..=9 {
                    ticks.push(Tick {
                        value: f64::from(m) * 10f64.powi(k),
                        label: String::new(),
                    });
                }
            }
        }
        Axis {
            lo: 10f64.powi(k0),
            hi: 10f64.powi(k1),
            scale: Scale::Log,
            ticks,
        }
    }

    /// Fraction `t` of the way from `lo` to `hi` (module docs); `None` for a value a log axis
    /// cannot show or a non-finite value.
    #[must_use]
    pub fn fraction(&self, v: f64) -> Option<f64> {
        if !v.is_finite() {
            return None;
        }
        match self.scale {
            Scale::Linear => Some((v - self.lo) / (self.hi - self.lo)),
            Scale::Log => (v > 0.0)
                .then(|| (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())),
        }
    }
}

/// `v` as `m.mmme±k` with as many digits as the spacing `d` needs.
fn scientific_label(v: f64, d: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (v.abs().log10().floor() - d.log10().floor()).clamp(0.0, 6.0) as usize;
    let s = format!("{v:.digits$e}");
    s
}

/// `10` followed by the exponent in superscript digits, for example `10⁻³`.
fn power_of_ten(k: i32) -> String {
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::from("10");
    if k < 0 {
        s.push('⁻');
    }
    for c in k.unsigned_abs().to_string().chars() {
        s.push(SUP[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// The data range of every series on one axis (`x` when `first`), leaving out what `scale`
/// cannot show.
fn data_range(chart: &Chart, first: bool, scale: Scale) -> Option<(f64, f64)> {
    let mut range: Option<(f64, f64)> = None;
    for s in &chart.series {
        for &(x, y) in s.points.iter().chain(s.band.iter().flatten()) {
            let v = if first { x } else { y };
            let other = if first { y } else { x };
            let other_scale = if first { chart.y_scale } else { chart.x_scale };
            let ok = |v: f64, sc: Scale| v.is_finite() && (sc == Scale::Linear || v > 0.0);
            if !ok(v, scale) || !ok(other, other_scale) {
                continue;
            }
            range = Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
        }
    }
    range
}

/// Share of the data range left free beyond the data at each end of an axis (on a log axis, of
/// the range in decades), so that nothing is drawn on the frame.
const MARGIN: f64 = 0.04;

fn make_axis(range: Option<(f64, f64)>, fixed: Option<(f64, f64)>, scale: Scale) -> Axis {
    let (a, b) = fixed.or(range).unwrap_or(match scale {
        Scale::Linear => (0.0, 1.0),
        Scale::Log => (1.0, 10.0),
    });
    let mut axis = match scale {
        Scale::Linear => Axis::linear(a, b, 6),
        Scale::Log => Axis::log(a, b),
    };
    let ends = match fixed {
        // A fixed range is kept exactly.
        Some((lo, hi)) if lo < hi && (scale == Scale::Linear || lo > 0.0) => Some((lo, hi)),
        Some(_) => None,
        None if b > a => Some(match scale {
            Scale::Linear => (a - MARGIN * (b - a), b + MARGIN * (b - a)),
            Scale::Log => {
                let span = b.log10() - a.log10();
                (
                    10f64.powf(a.log10() - MARGIN * span),
                    10f64.powf(b.log10() + MARGIN * span),
                )
            }
        }),
        None => None,
    };
    if let Some((lo, hi)) = ends {
        axis.lo = lo;
        axis.hi = hi;
        // Only ticks inside stay (or outside by rounding only).
        let inside = axis.clone();
        axis.ticks.retain(|t| {
            inside
                .fraction(t.value)
                .is_some_and(|f| (-1e-9..=1.0 + 1e-9).contains(&f))
        });
    }
    if scale == Scale::Log && axis.ticks.iter().filter(|t| !t.label.is_empty()).count() < 2 {
        // Less than two decades in view: label 1, 2 and 5 times each power of ten, or every
        // tick when that is still less than two labels.
        let nice_125 = |v: f64| {
            let m = v / 10f64.powf(v.log10().floor());
            [1.0, 2.0, 5.0, 10.0].iter().any(|n| (m - n).abs() < 1e-6)
        };
        let all = axis.ticks.iter().filter(|t| nice_125(t.value)).count() < 2;
        for t in &mut axis.ticks {
            if all || nice_125(t.value) {
                t.label = format_number(t.value);
            }
        }
    }
    axis
}

/// A short label for `v`: plain decimals between 0.001 and 10 000 (three significant digits at
/// most), else `m×10ᵏ`.
fn format_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        return if a == 0.0 { "0".into() } else { format!("{v}") };
    }
    let k = a.log10().floor() as i32;
    if (-3..4).contains(&k) {
        let decimals = (2 - k).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        return s;
    }
    let m = v / 10f64.powi(k);
    if (m.abs() - 1.0).abs() < 1e-9 {
        let sign = if v < 0.0 { "-" } else { "" };
        return format!("{sign}{}", power_of_ten(k));
    }
    let m = format!("{m:.2}");
    let m = m.trim_end_matches('0').trim_end_matches('.');
    format!("{m}×{}", power_of_ten(k))
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

/// Draws `chart` with the rasteriser settings `quality`.
///
/// # Panics
/// If a side is 0 or larger than [`super::MAX_SIDE`].
#[must_use]
pub fn draw_with(chart: &Chart, width: u32, height: u32, quality: Quality) -> Pixmap {
    assert!(check_size(width, height).is_ok(), "chart size out of range");
    let mut pixmap = Pixmap::new(width, height).expect("size checked");
    pixmap.fill(Colour::rgb(255, 255, 255).to_skia());
    let mut paint = Paint {
        anti_alias: quality.anti_alias,
        force_hq_pipeline: quality.force_hq_pipeline,
        ..Paint::default()
    };
    let (w, h) = (width as f32, height as f32);
    let s = (w.min(h) / 480.0).max(0.5);
    let px = (h.min(w) / 32.0).clamp(10.0, 40.0).round();
    let title_px = (1.2 * px).round();
    let (ascent, descent) = vertical_metrics(px);
    let (t_ascent, t_descent) = vertical_metrics(title_px);
    let pad = 0.6 * px;
    let tick = 0.4 * px;

    let x_axis = make_axis(
        data_range(chart, true, chart.x_scale),
        chart.x_range,
        chart.x_scale,
    );
    let y_axis = make_axis(
        data_range(chart, false, chart.y_scale),
        chart.y_range,
        chart.y_scale,
    );

    // Layout: title on top; y label and tick labels on the left; x tick labels and label below.
    let y_tick_w = y_axis
        .ticks
        .iter()
        .map(|t| text_width(&t.label, px))
        .fold(0.0f32, f32::max);
    let has_title = !chart.title.is_empty();
    // Legend: one entry per named series, in rows under the title.
    let colours: Vec<Colour> = chart
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| s.colour.unwrap_or(colour::SERIES[i % colour::SERIES.len()]))
        .collect();
    let sample = 1.8 * px;
    let entry_w = |s: &Series| sample + 0.4 * px + text_width(&s.name, px) + 1.2 * px;
    let mut rows: Vec<Vec<usize>> = Vec::new();
    let mut row_w = 0.0f32;
    for (i, series) in chart.series.iter().enumerate() {
        if series.name.is_empty() {
            continue;
        }
        let ew = entry_w(series);
        match rows.last_mut() {
            Some(row) if row_w + ew <= w - 2.0 * pad => {
                row.push(i);
                row_w += ew;
            }
            _ => {
                rows.push(vec![i]);
                row_w = ew;
            }
        }
    }
    let legend_line = (ascent + descent) * 1.2;
    let title_h = if has_title {
        t_ascent + t_descent + 0.5 * pad
    } else {
        0.0
    };
    let legend_top = pad + title_h;
    let top = legend_top + rows.len() as f32 * legend_line + 0.5 * pad;
    let left =
        pad + if chart.y_label.is_empty() {
            0.0
        } else {
            ascent + descent + pad
        } + y_tick_w
            + tick
            + 0.5 * pad;
    let bottom = h
        - pad
        - if chart.x_label.is_empty() {
            0.0
        } else {
            ascent + descent + 0.5 * pad
        }
        - (ascent + descent)
        - tick;
    // Room for the last x tick label to the right.
    let right = w
        - pad
        - 0.5
            * x_axis
                .ticks
                .last()
                .map_or(0.0, |t| text_width(&t.label, px));
    let (pw, ph) = ((right - left).max(1.0), (bottom - top).max(1.0));
    let to_px = |x: f64, y: f64| -> Option<(f32, f32)> {
        let tx = x_axis.fraction(x)?;
        let ty = y_axis.fraction(y)?;
        Some((left + tx as f32 * pw, bottom - ty as f32 * ph))
    };

    if has_title {
        draw_text(
            &mut pixmap,
            &chart.title,
            0.5 * (left + right),
            pad + t_ascent,
            title_px,
            colour::TEXT,
            Align::Centre,
        );
    }
    // Grid, ticks and tick labels.
    let grid = Colour::rgb(228, 231, 236);
    let minor_grid = Colour::rgb(242, 243, 246);
    let axis_colour = Colour::rgb(70, 74, 82);
    // Right end of the last x label and top of the last y label drawn (px).
    let mut last_x_label = f32::NEG_INFINITY;
    let mut last_y_label = f32::INFINITY;
    for t in &x_axis.ticks {
        let Some(f) = x_axis.fraction(t.value) else {
            continue;
        };
        let x = left + f as f32 * pw;
        let major = !t.label.is_empty() || x_axis.scale == Scale::Linear;
        let g = if major { grid } else { minor_grid };
        stroke_line(&mut pixmap, &mut paint, pt(x, top), pt(x, bottom), s, g);
        let len = if major { tick } else { 0.5 * tick };
        stroke_line(
            &mut pixmap,
            &mut paint,
            pt(x, bottom),
            pt(x, bottom + len),
            s,
            axis_colour,
        );
        let half = 0.5 * text_width(&t.label, px);
        if !t.label.is_empty() && x - half >= last_x_label + 0.5 * px {
            last_x_label = x + half;
            draw_text(
                &mut pixmap,
                &t.label,
                x,
                bottom + tick + ascent,
                px,
                colour::TEXT,
                Align::Centre,
            );
        }
    }
    for t in &y_axis.ticks {
        let Some(f) = y_axis.fraction(t.value) else {
            continue;
        };
        let y = bottom - f as f32 * ph;
        let major = !t.label.is_empty() || y_axis.scale == Scale::Linear;
        let g = if major { grid } else { minor_grid };
        stroke_line(&mut pixmap, &mut paint, pt(left, y), pt(right, y), s, g);
        let len = if major { tick } else { 0.5 * tick };
        stroke_line(
            &mut pixmap,
            &mut paint,
            pt(left - len, y),
            pt(left, y),
            s,
            axis_colour,
        );
        // Labels go upwards: the next one must end above this one's top.
        if !t.label.is_empty() && y + 0.5 * ascent <= last_y_label - 0.2 * px {
            last_y_label = y - 0.5 * ascent;
            draw_text(
                &mut pixmap,
                &t.label,
                left - tick - 0.3 * pad,
                y + 0.35 * ascent,
                px,
                colour::TEXT,
                Align::Right,
            );
        }
    }
    // Axis labels.
    if !chart.x_label.is_empty() {
        draw_text(
            &mut pixmap,
            &chart.x_label,
            left + 0.5 * pw,
            h - pad - descent,
            px,
            colour::TEXT,
            Align::Centre,
        );
    }
    if !chart.y_label.is_empty() {
        draw_text_vertical(
            &mut pixmap,
            &chart.y_label,
            pad + ascent,
            top + 0.5 * ph,
            px,
            colour::TEXT,
        );
    }

    // Series, clipped to the plot.
    let mut mask = Mask::new(width, height).expect("size checked");
    if let Some(rect) = Rect::from_xywh(left, top, pw, ph) {
        mask.fill_path(
            &PathBuilder::from_rect(rect),
            FillRule::Winding,
            false,
            Transform::identity(),
        );
    }
    for (series, &c) in chart.series.iter().zip(&colours) {
        if let Some(lower) = &series.band {
            // The polygon along the upper points and back along the lower ones.
            let mut pb = PathBuilder::new();
            let mut started = false;
            for &(x, y) in series.points.iter().chain(lower.iter().rev()) {
                if let Some((u, v)) = to_px(x, y)
                    && u.is_finite()
                    && v.is_finite()
                {
                    if started {
                        pb.line_to(u, v);
                    } else {
                        pb.move_to(u, v);
                        started = true;
                    }
                }
            }
            pb.close();
            if let Some(path) = pb.finish() {
                let mut fill = c.to_skia();
                fill.set_alpha(0.25);
                paint.set_color(fill);
                pixmap.fill_path(
                    &path,
                    &paint,
                    FillRule::Winding,
                    Transform::identity(),
                    Some(&mask),
                );
            }
        }
        if matches!(series.style, SeriesStyle::Line | SeriesStyle::LineAndPoints) {
            let mut pb = PathBuilder::new();
            let mut pen_down = false;
            for &(x, y) in &series.points {
                match to_px(x, y) {
                    Some((u, v)) if u.is_finite() && v.is_finite() => {
                        if pen_down {
                            pb.line_to(u, v);
                        } else {
                            pb.move_to(u, v);
                            pen_down = true;
                        }
                    }
                    _ => pen_down = false,
                }
            }
            if let Some(path) = pb.finish() {
                paint.set_color(c.to_skia());
                let stroke = Stroke {
                    width: 2.0 * s,
                    line_cap: LineCap::Round,
                    line_join: LineJoin::Round,
                    ..Stroke::default()
                };
                pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), Some(&mask));
            }
        }
        if matches!(
            series.style,
            SeriesStyle::Scatter | SeriesStyle::LineAndPoints
        ) {
            for &(x, y) in &series.points {
                if let Some((u, v)) = to_px(x, y)
                    && let Some(path) = PathBuilder::from_circle(u, v, 3.2 * s)
                {
                    paint.set_color(c.to_skia());
                    pixmap.fill_path(
                        &path,
                        &paint,
                        FillRule::Winding,
                        Transform::identity(),
                        Some(&mask),
                    );
                    paint.set_color(Colour::rgb(255, 255, 255).to_skia());
                    let stroke = Stroke {
                        width: 0.9 * s,
                        ..Stroke::default()
                    };
                    pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), Some(&mask));
                }
            }
        }
    }
    // Frame around the plot.
    if let Some(rect) = Rect::from_xywh(left, top, pw, ph) {
        paint.set_color(axis_colour.to_skia());
        let stroke = Stroke {
            width: s,
            ..Stroke::default()
        };
        pixmap.stroke_path(
            &PathBuilder::from_rect(rect),
            &paint,
            &stroke,
            Transform::identity(),
            None,
        );
    }
    // Legend rows, each centred over the plot.
    for (r, row) in rows.iter().enumerate() {
        let total: f32 = row.iter().map(|&i| entry_w(&chart.series[i])).sum::<f32>() - 1.2 * px;
        let mut x = (0.5 * (left + right) - 0.5 * total)
            .min(w - pad - total)
            .max(pad);
        let baseline = legend_top + ascent + r as f32 * legend_line;
        let mid = baseline - 0.35 * ascent;
        for &i in row {
            let series = &chart.series[i];
            let c = colours[i];
            if matches!(series.style, SeriesStyle::Line | SeriesStyle::LineAndPoints) {
                stroke_line(
                    &mut pixmap,
                    &mut paint,
                    pt(x, mid),
                    pt(x + sample, mid),
                    2.0 * s,
                    c,
                );
            }
            if matches!(
                series.style,
                SeriesStyle::Scatter | SeriesStyle::LineAndPoints
            ) && let Some(path) = PathBuilder::from_circle(x + 0.5 * sample, mid, 3.2 * s)
            {
                paint.set_color(c.to_skia());
                pixmap.fill_path(
                    &path,
                    &paint,
                    FillRule::Winding,
                    Transform::identity(),
                    None,
                );
            }
            draw_text(
                &mut pixmap,
                &series.name,
                x + sample + 0.4 * px,
                baseline,
                px,
                colour::TEXT,
                Align::Left,
            );
            x += entry_w(series);
        }
    }
    pixmap
}

fn pt(x: f32, y: f32) -> tiny_skia::Point {
    tiny_skia::Point::from_xy(x, y)
}

#[cfg(test)]
mod tests {
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
