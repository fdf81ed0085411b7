//! Lesson 8's charts: the scene's observable over time beside the recorded study's value
//! (`observable`), and the recorded resolution study (`resolution`): the sag at T against the
//! cloth's resolution, with every spring kind and without bend or shear springs.
//!
//! The studies take minutes; their output is recorded in the repository's `docs/studies/` and
//! `tests/lesson8.rs` checks the recording against the code (its cheapest levels re-run bit for
//! bit) and every number lesson 8 quotes against the recording. The app reads the same files,
//! built into the binary.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::Span;
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Widget};
use serde_json::Value;

use super::Theme;
use super::lesson_run::LessonRun;
use super::plots::{fit_title, number};
use crate::lesson::{Plot, Step};

/// The recorded `study resolution cloth-sphere`.
const RESOLUTION: &str = include_str!("../../docs/studies/resolution-cloth-sphere.json");
/// The recorded `advise jelly-bowl --tolerance 0.01`.
const ADVISE: &str = include_str!("../../docs/studies/advise-jelly-bowl.json");

/// The colours of the components and of the recorded values.
const COLOURS: [Color; 4] = [Color::Cyan, Color::LightRed, Color::Green, Color::Magenta];
const RECORDED: Color = Color::Yellow;

/// What a recorded study says of this step's body: where it comes from, at which time (s),
/// and the headline value of each observable component (as [`super::lesson_run::Observed`]
/// orders them; `None` where the recording has none).
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    pub source: String,
    pub time: f64,
    pub values: Vec<Option<f64>>,
}

/// The value of `key` in the step's `key=value` parameters.
fn param(step: &Step, key: &str) -> Option<f64> {
    step.params.iter().find_map(|s| {
        let (k, v) = s.split_once('=')?;
        (k.trim() == key).then(|| v.trim().parse().ok()).flatten()
    })
}

/// The headline of a recorded component value: a point's height, a length.
fn headline(v: &Value) -> Option<f64> {
    match v {
        Value::Array(p) => p.get(1).and_then(Value::as_f64),
        v => v.as_f64(),
    }
}

/// The resolution study's spring kinds of the step's body.
fn kinds(step: &Step) -> &'static str {
    if param(step, "bend_stiffness") == Some(0.0) {
        "no-bend"
    } else if param(step, "shear_stiffness") == Some(0.0) {
        "no-shear"
    } else {
        "all"
    }
}

/// The recorded study's value for the step's body, when a recording covers it: the
/// resolution study's level of the same n and spring kinds (its RK4 run), or the advise
/// search's converged reference on its scene at its own resolution.
#[must_use]
pub fn recorded(step: &Step) -> Option<Recorded> {
    let resolution: Value = serde_json::from_str(RESOLUTION).ok()?;
    if resolution["scene"].as_str() == Some(step.scene.as_str()) {
        let n = param(step, "n").or_else(|| resolution["base"].as_f64())?;
        let kinds = kinds(step);
        let run = resolution["runs"]
            .as_array()?
            .iter()
            .find(|r| r["n"].as_f64() == Some(n) && r["kinds"] == kinds)?;
        let values = run["run"]["observation"]["components"]
            .as_array()?
            .iter()
            .filter(|c| c["unit"] != "s")
            .map(|c| headline(&c["value"]))
            .collect();
        return Some(Recorded {
            source: format!("study n = {n}, RK4"),
            time: resolution["time"].as_f64()?,
            values,
        });
    }
    let advise: Value = serde_json::from_str(ADVISE).ok()?;
    let reference = &advise["reference"];
    if advise["scene"].as_str() == Some(step.scene.as_str())
        && step.params.is_empty()
        && reference["converged"] == true
    {
        let values = reference["observation"]["components"]
            .as_array()?
            .iter()
            .filter(|c| c["unit"] != "s")
            .map(|c| headline(&c["value"]))
            .collect();
        return Some(Recorded {
            source: "advise's converged RK4".into(),
            time: advise["time"].as_f64()?,
            values,
        });
    }
    None
}

/// The resolution study's recorded levels: per spring kind, (n, sag at T) in order of n.
fn levels() -> Vec<(&'static str, Vec<(f64, f64)>)> {
    let Ok(resolution) = serde_json::from_str::<Value>(RESOLUTION) else {
        return Vec::new();
    };
    let runs = resolution["runs"].as_array().cloned().unwrap_or_default();
    ["all", "no-bend", "no-shear"]
        .into_iter()
        .map(|kinds| {
            let points = runs
                .iter()
                .filter(|r| r["kinds"] == kinds)
                .filter_map(|r| {
                    let n = r["n"].as_f64()?;
                    let v = headline(&r["run"]["observation"]["components"][0]["value"])?;
                    Some((n, v))
                })
                .collect();
            (kinds, points)
        })
        .collect()
}

/// The instant the resolution study observes (s).
fn resolution_time() -> f64 {
    serde_json::from_str::<Value>(RESOLUTION)
        .ok()
        .and_then(|r| r["time"].as_f64())
        .unwrap_or(f64::NAN)
}

/// Draws `plot` (one of lesson 8's) of `run` in `area`.
pub fn render(plot: Plot, run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    match plot {
        Plot::Resolution => render_resolution(run, theme, area, buf),
        _ => render_observable(run, theme, area, buf),
    }
}

/// Lower and upper bounds of `values`, widened by 5 % (and around a single value).
fn bounds(values: impl Iterator<Item = f64>) -> [f64; 2] {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return [0.0, 1.0];
    }
    let pad = ((hi - lo) * 0.05).max(1e-3 * hi.abs().max(1e-3));
    [lo - pad, hi + pad]
}

fn axis_labels(b: [f64; 2], theme: Theme) -> Vec<Span<'static>> {
    axis_labels_unit(b, "", theme)
}

/// The two ends of an axis, the unit after the last.
fn axis_labels_unit(b: [f64; 2], unit: &str, theme: Theme) -> Vec<Span<'static>> {
    vec![
        Span::styled(number(b[0]), theme.dim()),
        Span::styled(format!("{}{unit}", number(b[1])), theme.dim()),
    ]
}

fn render_observable(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let observed = run.observed();
    let reference = recorded(run.step());
    let now = run.sim().time();
    let horizon = reference.as_ref().map_or(now, |r| r.time).max(now).max(0.1);
    let curves: Vec<Vec<(f64, f64)>> = (0..observed.names.len())
        .map(|i| observed.samples.iter().map(|(t, v)| (*t, v[i])).collect())
        .collect();
    let marks: Vec<Vec<(f64, f64)>> = (0..observed.names.len())
        .map(|i| {
            reference
                .as_ref()
                .and_then(|r| r.values.get(i).copied().flatten())
                .map(|v| vec![(reference.as_ref().map_or(0.0, |r| r.time), v)])
                .unwrap_or_default()
        })
        .collect();
    let mut title = vec![Span::styled("observable", theme.fg(Color::Cyan))];
    if let Some((t, values)) = observed.latest() {
        // The names in their curves' colours: the title is the legend (a legend box inside
        // the chart would cover the curves).
        for (i, (name, v)) in observed.names.iter().zip(values).enumerate() {
            let sep = if i == 0 { " " } else { " · " };
            title.push(Span::styled(
                format!("{sep}{name} {}", number(*v)),
                theme.fg(COLOURS[i % COLOURS.len()]),
            ));
        }
        title.push(Span::styled(format!(" · t {} s", number(*t)), theme.dim()));
    }
    if let Some(r) = &reference {
        title.push(Span::styled(
            format!(" · ■ {}", r.source),
            theme.fg(RECORDED),
        ));
    }
    let title = fit_title(title, area.width);
    let mut datasets = Vec::new();
    for (i, (curve, name)) in curves.iter().zip(&observed.names).enumerate() {
        datasets.push(
            Dataset::default()
                .name(name.clone())
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(theme.fg(COLOURS[i % COLOURS.len()]))
                .data(curve),
        );
    }
    let source = reference.as_ref().map(|r| r.source.clone());
    for mark in marks.iter().filter(|m| !m.is_empty()) {
        datasets.push(
            Dataset::default()
                .name(source.clone().unwrap_or_default())
                .marker(Marker::Block)
                .graph_type(GraphType::Scatter)
                .style(theme.fg(RECORDED))
                .data(mark),
        );
    }
    let x = [0.0, horizon];
    let y = bounds(
        curves
            .iter()
            .chain(&marks)
            .flat_map(|c| c.iter().map(|p| p.1)),
    );
    let chart = Chart::new(datasets)
        .block(Block::bordered().title(title))
        // The unit on the last label ("3 s"): an axis title would sit on the data's last row.
        .x_axis(
            Axis::default()
                .bounds(x)
                .labels(axis_labels_unit(x, " s", theme)),
        )
        .y_axis(Axis::default().bounds(y).labels(axis_labels(y, theme)))
        .legend_position(None);
    chart.render(area, buf);
}

fn render_resolution(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let levels = levels();
    let step = run.step();
    let here = param(step, "n");
    let colours = [Color::Cyan, Color::Green, Color::LightRed];
    let mut datasets = Vec::new();
    for (i, (kinds, points)) in levels.iter().enumerate() {
        datasets.push(
            Dataset::default()
                .name(format!("sag, {kinds}"))
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(theme.fg(colours[i % colours.len()]))
                .data(points),
        );
    }
    let x = bounds(levels.iter().flat_map(|l| l.1.iter().map(|p| p.0)));
    let y = bounds(levels.iter().flat_map(|l| l.1.iter().map(|p| p.1)));
    // The title is the legend: each curve's springs in its colour.
    let mut title = vec![Span::styled("sag:", theme.fg(Color::Cyan))];
    for (i, (kinds, _)) in levels.iter().enumerate() {
        title.push(Span::styled(
            format!(" {kinds}"),
            theme.fg(colours[i % colours.len()]),
        ));
    }
    title.push(Span::raw(format!(
        " · resolution: sag (m) at {} s against n",
        number(resolution_time())
    )));
    title.push(Span::raw(" · recorded study"));
    title.push(Span::styled(
        here.map_or(String::new(), |n| format!(" · this step n = {n}")),
        theme.dim(),
    ));
    let title = fit_title(title, area.width);
    let chart = Chart::new(datasets)
        .block(Block::bordered().title(title))
        .x_axis(
            Axis::default()
                .bounds(x)
                .labels(axis_labels_unit(x, "", theme)),
        )
        .y_axis(Axis::default().bounds(y).labels(axis_labels(y, theme)))
        .legend_position(None);
    chart.render(area, buf);
}
