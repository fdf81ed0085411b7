//! The plots beside the scene: energy over time, the oscillator beside its exact solution, the
//! largest speed and the oscillator's error, drawn as braille charts.
//!
//! Samples are taken on a grid of simulated time (never wall time), so the same run gives the
//! same plot whatever the frame rate.

mod axis;
mod history;
mod series;
mod study;

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;

use super::Theme;
use crate::lesson::Plot;
use crate::physics::Method;
use series::render_one;

pub use axis::number;
pub use history::{Bin, History, Oscillator, Sample};
pub use study::Studies;

/// Draws the charts for `plots` side by side in `area`; `shown` picks the methods of the study
/// charts (by index into [`Method::ALL`](crate::physics::Method::ALL)).
#[allow(clippy::too_many_arguments)]
pub fn render(
    plots: &[Plot],
    history: &History,
    oscillator: Option<&Oscillator>,
    studies: &Studies,
    shown: [bool; Method::COUNT],
    now: f64,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    if plots.is_empty() || area.width == 0 {
        return;
    }
    let count = plots.len() as u16;
    let width = area.width / count;
    for (i, plot) in plots.iter().enumerate() {
        let i = i as u16;
        let w = if i + 1 == count {
            area.width - width * i
        } else {
            width
        };
        let rect = Rect::new(area.x + width * i, area.y, w, area.height);
        let view = View {
            history,
            oscillator,
            studies,
            shown,
            now,
            theme,
        };
        render_one(*plot, &view, rect, buf);
    }
}

/// What every chart may draw from.
struct View<'a> {
    history: &'a History,
    oscillator: Option<&'a Oscillator>,
    studies: &'a Studies,
    shown: [bool; Method::COUNT],
    now: f64,
    theme: Theme,
}
