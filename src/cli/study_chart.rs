//! The PNG charts of `study convergence` and `study work-precision`: error against time step, or
//! error against cost, on log-log axes, one line with markers per method.

use std::path::Path;

use anyhow::Context;

use crate::render::chart::{self, Chart, Series, SeriesStyle};
use crate::study::convergence::ConvergenceReport;

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
