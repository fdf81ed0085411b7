//! When the raster view sends the plots as a picture: only when what they show changed, at most
//! every [`PICTURE_PERIOD`] while the simulation runs (so the charts cost a few frames a second
//! at most), at once when it is paused. Where the picture goes and whether the one in the
//! encoder still fits the screen.

use std::time::Instant;

use ratatui::layout::Rect;

use super::Theme;
use super::lesson_run::LessonRun;
use super::lesson_view;
use super::plots::picture::{PICTURE_PERIOD, Picture, picture_area};
use super::plots::{self};

/// What was last sent.
#[derive(Clone, Copy, Debug, Default)]
pub struct ChartFeed {
    key: Option<u64>,
    at: Option<Instant>,
}

/// The plots' data of `run` for `theme`.
fn data(run: &LessonRun, theme: Theme) -> plots::Data<'_> {
    plots::Data {
        history: run.history(),
        oscillator: run.oscillator(),
        studies: run.studies(),
        shown: run.shown_methods(),
        now: run.sim().time(),
        theme,
    }
}

impl ChartFeed {
    /// The picture to send with the next job when the lesson screen fills `screen`: `None`
    /// when nothing changed, when the last one is younger than [`PICTURE_PERIOD`] and the run
    /// goes on, or when no plot is drawn as a picture.
    pub fn due(
        &mut self,
        run: &LessonRun,
        screen: Rect,
        theme: Theme,
        cell: (u16, u16),
        now: Instant,
    ) -> Option<Picture> {
        let (shown, area) = lesson_view::plots_area(run, screen)?;
        let d = data(run, theme);
        let key = d.picture_key(&shown, area);
        if self.key == Some(key)
            || (run.is_running() && self.at.is_some_and(|t| now - t < PICTURE_PERIOD))
        {
            return None;
        }
        let picture = d.picture(&shown, area, cell)?;
        self.key = Some(key);
        self.at = Some(now);
        Some(picture)
    }

    /// Forgets what was sent (a new lesson, a new size: the next picture goes at once).
    pub fn reset(&mut self) {
        *self = ChartFeed::default();
    }
}

/// The cells the plots' picture covers when the lesson screen fills `screen`, if any.
#[must_use]
pub fn area(run: &LessonRun, screen: Rect) -> Option<Rect> {
    let (shown, area) = lesson_view::plots_area(run, screen)?;
    picture_area(&shown, area)
}
