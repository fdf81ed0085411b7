//! The PNG charts of `study convergence` and `study work-precision`: error against time step, or
//! error against cost, on log-log axes, one line with markers per method.

use std::path::Path;

use anyhow::Context;

use crate::render::chart::{self, Chart, Series, SeriesStyle};
use crate::study::convergence::ConvergenceReport;
use crate::study::resolution::{Kinds, ResolutionReport};

/// Chart size (px).
const WIDTH: u32 = 800;
const HEIGHT: u32 = 560;

/// The study's log-log chart: `error (m)` against `dt (s)` (convergence) or against force
/// evaluations (work-precision). Points whose run diverged are left out; the legend gives each
/// method's fitted order.
#[must_use]
pub fn chart(report: &ConvergenceReport, work_precision: bool) -> Chart {
    let (title, x_label) = if work_precision {
        (
            format!("Work-precision: {} at t = {} s", report.scene, report.time),
            "cost: force evaluations",
        )
    } else {
        (
            format!("Convergence: {} at t = {} s", report.scene, report.time),
            "time step dt (s)",
        )
    };
    let mut c = Chart::new(title, x_label, "error max |x - x_ref| (m)").log_log();
    for m in &report.methods {
        let points = m
            .points
            .iter()
            .filter_map(|p| {
                let x = if work_precision {
                    p.force_evals as f64
                } else {
                    p.dt
                };
                p.error.map(|e| (x, e))
            })
            .collect();
        let name = match m.order {
            Some(order) => format!("{} (order {order:.2})", m.method.name()),
            None => m.method.name().to_string(),
        };
        c = c.with(Series::line(name, points).with_style(SeriesStyle::LineAndPoints));
    }
    c
}

/// Draws the study's chart (see [`chart`]) into `path` as an 800×560 PNG.
///
/// # Errors
/// The file cannot be written.
pub fn save(report: &ConvergenceReport, work_precision: bool, path: &Path) -> anyhow::Result<()> {
    chart::save_png(&chart(report, work_precision), path, WIDTH, HEIGHT)
        .with_context(|| format!("--png {}: cannot write the chart", path.display()))
}

/// The resolution study's log-log chart against particle count: each level's difference from
/// the finest and from the next level (every spring kind), each variant's difference from every
/// kind at the same level, and the tolerance as a horizontal line. Zero and diverged
/// differences are left out (a log axis has no room for them).
#[must_use]
pub fn resolution_chart(report: &ResolutionReport) -> Chart {
    let unit = if report
        .components
        .iter()
        .any(|c| c.1 == crate::study::observe::Unit::Second)
    {
        "m or s"
    } else {
        "m"
    };
    let mut c = Chart::new(
        format!(
            "Resolution: {} at t = {} s ({})",
            report.scene, report.time, report.method
        ),
        "particles",
        format!("difference ({unit})"),
    )
    .log_log();
    let points =
        |kinds: Kinds, pick: &dyn Fn(&crate::study::resolution::LevelRun) -> Option<f64>| {
            report
                .runs
                .iter()
                .filter(|r| r.kinds == kinds)
                .filter_map(|r| {
                    pick(r)
                        .filter(|d| *d > 0.0 && d.is_finite())
                        .map(|d| (r.particles as f64, d))
                })
                .collect::<Vec<_>>()
        };
    let series = [
        (
            "from the finest level",
            points(Kinds::All, &|r| r.change_finest.as_ref().map(|d| d.worst())),
        ),
        (
            "to the next level",
            points(Kinds::All, &|r| r.change_next.as_ref().map(|d| d.worst())),
        ),
        (
            "without bend vs all kinds",
            points(Kinds::NoBend, &|r| {
                r.change_kinds.as_ref().map(|d| d.worst())
            }),
        ),
        (
            "without shear vs all kinds",
            points(Kinds::NoShear, &|r| {
                r.change_kinds.as_ref().map(|d| d.worst())
            }),
        ),
    ];
    let mut xs: Vec<f64> = report.runs.iter().map(|r| r.particles as f64).collect();
    xs.sort_by(f64::total_cmp);
    for (name, p) in series {
        if !p.is_empty() {
            c = c.with(Series::line(name, p).with_style(SeriesStyle::LineAndPoints));
        }
    }
    if let (Some(&lo), Some(&hi)) = (xs.first(), xs.last()) {
        c = c.with(Series::line(
            format!("tolerance X = {}", report.tolerance),
            vec![(lo, report.tolerance), (hi, report.tolerance)],
        ));
    }
    c
}

/// Draws [`resolution_chart`] into `path` as an 800×560 PNG.
///
/// # Errors
/// The file cannot be written.
pub fn save_resolution(report: &ResolutionReport, path: &Path) -> anyhow::Result<()> {
    chart::save_png(&resolution_chart(report), path, WIDTH, HEIGHT)
        .with_context(|| format!("--png {}: cannot write the chart", path.display()))
}
