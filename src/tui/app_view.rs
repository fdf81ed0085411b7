//! Drawing the app: the menu or the lesson screen, the help over it, the scene pane's painter per view.

use ratatui::buffer::Buffer;
use ratatui::layout::{Alignment, Rect};
use ratatui::style::Color;
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget, Wrap};

use super::raster::Encoder;
use super::sim_view::Painter;

use super::{
    App, LessonRun, MIN_SIZE, Screen, Theme, ViewMode, halfblocks, help, lesson_view, menu, raster,
    sim_view,
};

impl Widget for &App {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let theme = self.theme;
        if area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1 {
            too_small(area, buf, theme);
            return;
        }
        match &self.screen {
            Screen::Menu => menu::render(self, area, buf),
            Screen::Lesson(run) => {
                let label = self.view_label();
                let canvas = lesson_view::render(
                    run,
                    self.fps,
                    &label,
                    theme,
                    &ScenePainter { app: self },
                    area,
                    buf,
                );
                self.canvas_area.set(canvas);
                show_picture(self, run, area, buf);
                super::homework_view::render(self, run, theme, canvas, buf);
            }
        }
        if self.help {
            let menu = matches!(self.screen, Screen::Menu);
            let shown = help::render(menu, theme, area, buf, self.help_scroll.get());
            self.help_scroll.set(shown);
        }
    }
}

/// The stamp of a raster job: the lesson opened (`opened`, high bits) and the run's version.
pub(super) fn raster_stamp(opened: u64, version: u64) -> u64 {
    (opened << 40) | (version & ((1 << 40) - 1))
}

/// In the raster view, the plots' picture over their braille drawing when it fits the screen
/// as it is now (else the braille plots stay).
fn show_picture(app: &App, run: &LessonRun, area: Rect, buf: &mut Buffer) {
    if app.view != ViewMode::Raster || app.help {
        return;
    }
    if let Some(p) = app.encoder.as_ref().and_then(Encoder::latest_picture)
        && p.stamp >> 40 == app.opened
        && super::chart_feed::area(run, area) == Some(p.area)
    {
        raster::show(&p.encoded, p.area, buf);
    }
}

/// Draws the scene pane's content in the app's view.
struct ScenePainter<'a> {
    app: &'a App,
}

impl Painter for ScenePainter<'_> {
    fn paint(&self, run: &LessonRun, theme: Theme, inner: Rect, buf: &mut Buffer) {
        let app = self.app;
        if app.view == ViewMode::Raster
            && let Some(frame) = app.encoder.as_ref().and_then(Encoder::latest)
            && frame.cells == ratatui::layout::Size::new(inner.width, inner.height)
            && frame.stamp >> 40 == app.opened
        {
            raster::show(&frame.encoded, inner, buf);
            return;
        }
        match app.view {
            ViewMode::Braille => sim_view::Braille.paint(run, theme, inner, buf),
            // The raster view shows half-blocks until its first frame is encoded.
            ViewMode::HalfBlocks | ViewMode::Raster => {
                let pixmap = app.pane.borrow_mut().draw(
                    &run.sim().scene,
                    run.generation(),
                    run.camera(),
                    run.spring_filter(),
                    (u32::from(inner.width), 2 * u32::from(inner.height)),
                    None,
                );
                halfblocks::render(&pixmap, app.colour, inner, buf);
            }
        }
    }
}

fn too_small(area: Rect, buf: &mut Buffer, theme: Theme) {
    let text = vec![
        Line::from(format!(
            "The terminal is {}×{}; springlab needs at least {}×{}.",
            area.width, area.height, MIN_SIZE.0, MIN_SIZE.1
        )),
        Line::from("Enlarge the window, or press q to go back."),
    ];
    let top = area.height.saturating_sub(2) / 2;
    let rect = Rect::new(area.x, area.y + top, area.width, area.height - top);
    Paragraph::new(text)
        .alignment(Alignment::Center)
        .wrap(Wrap { trim: true })
        .style(theme.fg(Color::Yellow))
        .render(rect, buf);
}
