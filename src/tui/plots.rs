//! The plots beside the scene: energy over time, the oscillator beside its exact solution, the
//! largest speed and the oscillator's error, drawn as braille charts.
//!
//! Samples are taken on a grid of simulated time (never wall time), so the same run gives the
//! same plot whatever the frame rate.

mod axis;
mod history;
pub mod picture;
mod series;
mod study;

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;

use super::Theme;
use crate::lesson::Plot;
use crate::physics::Method;
use series::render_one;

pub use axis::{fit_title, number};
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
    for (plot, rect) in plots.iter().zip(picture::plot_rects(plots.len(), area)) {
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

/// What the plots draw from: the run's history, the oscillator, the studies, the methods shown
/// (by index into [`Method::ALL`](crate::physics::Method::ALL)), the present time and the theme.
#[derive(Clone, Copy)]
pub struct Data<'a> {
    /// The sampled run.
    pub history: &'a History,
    /// The oscillator and its exact motion, when the scene is one.
    pub oscillator: Option<&'a Oscillator>,
    /// Lesson 7's studies.
    pub studies: &'a Studies,
    /// The methods the study charts show.
    pub shown: [bool; Method::COUNT],
    /// Simulated time now (s).
    pub now: f64,
    /// The terminal's theme.
    pub theme: Theme,
}

impl Data<'_> {
    fn view(&self) -> View<'_> {
        View {
            history: self.history,
            oscillator: self.oscillator,
            studies: self.studies,
            shown: self.shown,
            now: self.now,
            theme: self.theme,
        }
    }

    /// The plots of `plots` in `area` that the raster view draws as a picture, `cell` pixels a
    /// cell (see [`picture`]).
    #[must_use]
    pub fn picture(
        &self,
        plots: &[Plot],
        area: Rect,
        cell: (u16, u16),
    ) -> Option<picture::Picture> {
        picture::picture(plots, &self.view(), area, cell)
    }

    /// A number that changes when the picture of `plots` in `area` would.
    #[must_use]
    pub fn picture_key(&self, plots: &[Plot], area: Rect) -> u64 {
        picture::key(plots, &self.view(), area)
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
