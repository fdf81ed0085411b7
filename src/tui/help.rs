//! The help overlay (`?`): every key, on top of the screen.

use ratatui::buffer::Buffer;
use ratatui::crossterm::event::KeyCode;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Widget};

use super::{Theme, markdown};

/// The controls: `(keys, what they do)`; an empty key starts a section.
pub const LESSON_KEYS: &[(&str, &str)] = &[
    ("", "Running"),
    ("space", "run / pause"),
    ("s", "one step (pauses)"),
    (
        "r",
        "back to t = 0 and the first view (keeps method, dt, k, pins)",
    ),
    (
        "R",
        "the step as it opened: its method, dt, k, pins and view, at t = 0",
    ),
    (
        "m",
        "choose a method: its letter or number (listed), or Enter; Tab: one body",
    ),
    (
        "+ / -",
        "dt × 2 / ÷ 2 (the status line shows the method's limit)",
    ),
    ("] / [", "cap on steps per frame × 2 / ÷ 2"),
    ("> / <", "speed × 2 / ÷ 2 (simulated s per wall s)"),
    ("", "Springs, damping and pins"),
    ("K / k", "stiffness × 1.5 / ÷ 1.5, every spring"),
    ("D / d", "damping × 1.5 / ÷ 1.5 (from 1 % of critical)"),
    (
        "A / a",
        "air drag on every particle × 2 / ÷ 2 (from c/m = 0.25 1/s)",
    ),
    (
        "G / g",
        "Verlet's damping γ per step × 10 / ÷ 10 (from 5e-5)",
    ),
    (
        "J / j",
        "projection passes per step × 2 / ÷ 2 (Verlet, XPBD)",
    ),
    ("1 – 4", "pin / free a cloth corner"),
    (
        "mouse",
        "drag a particle (held still); drag empty space: pan",
    ),
    ("", "Predictions and charts"),
    ("1 – 6", "answer a prediction (before the run)"),
    (
        "1 – 9 / x",
        "show / hide a method in lesson 7's charts / x(t) vs exact: whole run",
    ),
    (
        "Tab",
        "the step's next plot, where only one fits (80 columns)",
    ),
    (
        "+D",
        "energy plot: total + dissipated, flat for an exact method",
    ),
    (
        "res",
        "energy plot: E + D - E0, the method's own energy error",
    ),
    ("", "View"),
    ("arrows", "orbit the camera; Shift + arrows: pan"),
    ("i / o", "zoom in / out (also the mouse wheel)"),
    (
        "f / c",
        "follow the bodies on / off; back to the first view",
    ),
    ("v", "view: raster (graphics), half-blocks, braille"),
    ("t", "springs shown: all, struct, shear, bend, none"),
    ("PgUp/PgDn", "scroll the step's text; h / l: code sideways"),
    ("e", "export the view as PNG"),
    ("", "Lesson"),
    ("n / p", "next / previous step (n on the last: next lesson)"),
    ("q / Esc", "back to the menu"),
    ("Ctrl-C", "quit"),
];

/// The menu's keys.
pub const MENU_KEYS: &[(&str, &str)] = &[
    ("", "Menu"),
    ("↑ / ↓", "choose a lesson"),
    ("Enter", "open it"),
    ("1 – 9", "open lesson N"),
    ("q / Esc", "quit"),
];

/// Where the overlay is scrolled to, and what its last drawing showed: `top` is the first of
/// its `total` rows on screen, `shown` how many fit. On a terminal too short for every key
/// (80 × 24) the rows scroll; on a tall one everything shows and any key closes the overlay.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Scroll {
    /// The first row shown.
    pub top: u16,
    /// Rows shown (the last drawing's; 0 before the first).
    pub shown: u16,
    /// Rows in all.
    pub total: u16,
}

impl Scroll {
    /// True when the rows do not all fit.
    #[must_use]
    pub fn overflows(self) -> bool {
        self.total > self.shown
    }

    /// The scroll after `key` when it scrolls the overlay (↑/↓, PgUp/PgDn, Home/End,
    /// only while the rows do not all fit); `None` when the key closes it.
    #[must_use]
    pub fn after(self, key: KeyCode) -> Option<Scroll> {
        if !self.overflows() {
            return None;
        }
        let last = self.total - self.shown;
        let page = self.shown.saturating_sub(1).max(1);
        let top = match key {
            KeyCode::Down => self.top.saturating_add(1),
            KeyCode::Up => self.top.saturating_sub(1),
            KeyCode::PageDown => self.top.saturating_add(page),
            KeyCode::PageUp => self.top.saturating_sub(page),
            KeyCode::Home => 0,
            KeyCode::End => last,
            _ => return None,
        };
        Some(Scroll {
            top: top.min(last),
            ..self
        })
    }
}

/// Draws the overlay for the menu or for a lesson in the middle of `area`, scrolled to
/// `scroll.top` (clamped); returns what it showed.
pub fn render(menu: bool, theme: Theme, area: Rect, buf: &mut Buffer, scroll: Scroll) -> Scroll {
    let keys = if menu { MENU_KEYS } else { LESSON_KEYS };
    let key_style = theme.fg(Color::Cyan).add_modifier(Modifier::BOLD);
    let head_style = Style::new()
        .add_modifier(Modifier::BOLD)
        .patch(theme.fg(Color::Yellow));
    // Inside the border, with a column to spare on each side; the descriptions wrap beside
    // the key column.
    let wrap_width = area.width.saturating_sub(4).max(20);
    let indent = " ".repeat(12);
    // Each key's rows: the key (two spaces, padded to ten), then its description wrapped
    // beside that column.
    let entries: Vec<(bool, Vec<Line>)> = keys
        .iter()
        .map(|&(key, what)| {
            if key.is_empty() {
                return (false, vec![Line::from(Span::styled(what, head_style))]);
            }
            let mut rows =
                markdown::wrap_hanging(what, wrap_width, &format!("  {key:<10}"), &indent, theme);
            if let Some(first) = rows.first_mut().and_then(|row| row.spans.first_mut()) {
                first.style = key_style;
            }
            (true, rows)
        })
        .collect();
    let rows = |headings: bool| -> usize {
        entries
            .iter()
            .filter(|(key, _)| headings || *key)
            .map(|(_, rows)| rows.len())
            .sum()
    };
    let note = markdown::wrap_text(
        "limit: the method's largest stable dt here, dampers and drag included.",
        wrap_width,
        theme,
    );
    // Section headings and the note only when everything fits with them (and the closing
    // line, and the border).
    let note_rows = if menu { 0 } else { 1 + note.len() };
    let roomy = rows(true) + note_rows + 3 <= usize::from(area.height);
    let mut lines: Vec<Line> = entries
        .into_iter()
        .filter(|(key, _)| roomy || *key)
        .flat_map(|(_, rows)| rows)
        .collect();
    if !menu && roomy {
        lines.push(Line::from(""));
        lines.extend(note.into_iter().map(|line| line.style(theme.dim())));
    }
    // Rows for the text between the border and the closing line.
    let total = lines.len() as u16;
    let fit = area.height.saturating_sub(3);
    let shown = total.min(fit);
    let top = scroll.top.min(total - shown);
    let closing = if total > shown {
        format!(
            "rows {}–{} of {total} · ↑/↓ PgUp/PgDn scroll · any other key closes",
            top + 1,
            top + shown
        )
    } else {
        "any key closes this help".to_owned()
    };
    let mut lines: Vec<Line> = lines
        .into_iter()
        .skip(usize::from(top))
        .take(usize::from(shown))
        .collect();
    lines.push(Line::from(Span::styled(closing, theme.dim())));
    let width = lines
        .iter()
        .map(Line::width)
        .max()
        .unwrap_or(0)
        .min(usize::from(area.width.saturating_sub(4))) as u16
        + 4;
    let height = (lines.len() as u16 + 2).min(area.height);
    let rect = Rect::new(
        area.x + (area.width.saturating_sub(width)) / 2,
        area.y + (area.height.saturating_sub(height)) / 2,
        width.min(area.width),
        height,
    );
    Clear.render(rect, buf);
    Paragraph::new(lines)
        .block(
            Block::bordered()
                .title(" springlab keys ")
                .border_style(theme.fg(Color::Cyan)),
        )
        .render(rect, buf);
    Scroll { top, shown, total }
}
