//! The PNG charts of `study convergence` and `study work-precision` (needs the render module).

use std::path::Path;

use crate::study::convergence::ConvergenceReport;

/// Draws the study's log-log chart into `path`.
///
/// # Errors
/// Always, until the chart renderer lands.
pub fn save(_report: &ConvergenceReport, _work_precision: bool, path: &Path) -> anyhow::Result<()> {
    anyhow::bail!(
        "--png {}: charts need the render module, which is not built yet",
        path.display()
    )
}
