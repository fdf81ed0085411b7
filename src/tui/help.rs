//! The help overlay (`?`): every key, on top of the screen.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Widget};

use super::Theme;

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
        "1 – 8 / x",
        "show / hide a method in lesson 7's charts / x(t) vs exact: whole run",
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

/// Draws the overlay for the menu or for a lesson in the middle of `area`.
pub fn render(menu: bool, theme: Theme, area: Rect, buf: &mut Buffer) {
    let keys = if menu { MENU_KEYS } else { LESSON_KEYS };
    let key_style = theme.fg(Color::Cyan).add_modifier(Modifier::BOLD);
    let head_style = Style::new()
        .add_modifier(Modifier::BOLD)
        .patch(theme.fg(Color::Yellow));
    // Section headings and the note only when the terminal is tall enough for them.
    let roomy = keys.len() as u16 + 5 <= area.height;
    let mut lines: Vec<Line> = Vec::new();
    for (key, what) in keys {
        if key.is_empty() {
            if !roomy {
                continue;
            }
            lines.push(Line::from(Span::styled(*what, head_style)));
        } else {
            lines.push(Line::from(vec![
                Span::styled(format!("  {key:<10}"), key_style),
                Span::raw(*what),
            ]));
        }
    }
    if !menu && roomy {
        lines.push(Line::from(""));
        lines.push(Line::from(Span::styled(
            "limit: the method's largest stable dt here, dampers and drag included.",
            theme.dim(),
        )));
    }
    lines.push(Line::from(Span::styled(
        "any key closes this help",
        theme.dim(),
    )));
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
}
