//! The lesson menu: number, title and summary of each lesson; a lesson that failed to load shows
//! its error (file and line) greyed out instead.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use super::{App, markdown};

/// Draws the menu of `app` into `area`.
pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let theme = app.theme;
    // A message wraps to at most five rows (the path of a progress file kept aside is long).
    let message_lines: Vec<Line> = app.menu_message().map_or_else(Vec::new, |m| {
        markdown::wrap_hanging(m, area.width.saturating_sub(1), " ", " ", theme)
            .into_iter()
            .map(|l| l.patch_style(theme.fg(Color::Yellow)))
            .take(5)
            .collect()
    });
    let [title, list, message, hints] = Layout::vertical([
        Constraint::Length(3),
        Constraint::Fill(1),
        Constraint::Length(message_lines.len().max(1) as u16),
        Constraint::Length(1),
    ])
    .areas(area);
    let bold = Style::new().add_modifier(Modifier::BOLD);
    Paragraph::new(vec![
        Line::from(Span::styled(
            " springlab · lessons",
            bold.patch(theme.fg(Color::Cyan)),
        )),
        Line::from(Span::styled(
            " Mass-spring systems, the methods that move them, and where each one fails.",
            theme.dim(),
        )),
    ])
    .render(title, buf);

    let width = list.width.saturating_sub(8);
    let entries: Vec<Vec<Line>> = app
        .lessons()
        .iter()
        .enumerate()
        .map(|(i, lesson)| {
            let selected = i == app.selected();
            let pointer = if selected { " ▸ " } else { "   " };
            let mut lines = Vec::new();
            match lesson {
                Ok(l) => {
                    let mut head = bold;
                    if selected {
                        head = head.add_modifier(Modifier::REVERSED);
                    }
                    let per_step = app
                        .lesson_steps_done(i)
                        .unwrap_or_else(|| vec![false; l.steps.len()]);
                    let (done, steps) = (per_step.iter().filter(|d| **d).count(), per_step.len());
                    let mark = if done == steps && steps > 0 {
                        Span::styled(
                            " ✓ ",
                            theme.fg(Color::LightGreen).add_modifier(Modifier::BOLD),
                        )
                    } else {
                        Span::raw("   ")
                    };
                    // One mark per step: ✓ done (opened, goal met, prediction made), · not yet.
                    let strip: Vec<Span> = per_step
                        .iter()
                        .map(|&d| {
                            if d {
                                Span::styled("✓", theme.fg(Color::LightGreen))
                            } else {
                                Span::styled("·", theme.dim())
                            }
                        })
                        .collect();
                    let command = match app.lessons_dir() {
                        Some(dir) => {
                            format!("springlab --lessons {} lesson {}", dir.display(), l.slug)
                        }
                        None => format!("springlab lesson {}", l.slug),
                    };
                    let mut head = Line::from(
                        vec![
                            Span::styled(pointer, theme.fg(Color::Yellow)),
                            Span::styled(format!("{:>2}. {}", l.number, l.title), head),
                            mark,
                        ]
                        .into_iter()
                        .chain(strip)
                        .chain([Span::styled(format!(" {done}/{steps} steps"), theme.dim())])
                        .collect::<Vec<_>>(),
                    );
                    // The command to open it, when it fits whole: a command cut short at the
                    // edge would be one that does not work.
                    let open = Span::styled(format!(" · `{command}`"), theme.dim());
                    if head.width() + open.width() <= usize::from(list.width) {
                        head.push_span(open);
                    }
                    lines.push(head);
                    for line in markdown::wrap_text(&l.summary, width, theme) {
                        let mut spans = vec![Span::raw("       ")];
                        spans.extend(line.spans);
                        lines.push(Line::from(spans));
                    }
                }
                Err(e) => {
                    let mut head = theme.dim();
                    if selected {
                        head = head.add_modifier(Modifier::REVERSED);
                    }
                    lines.push(Line::from(vec![
                        Span::styled(pointer, theme.fg(Color::Yellow)),
                        Span::styled(" !  this lesson has an error:", head),
                    ]));
                    for line in markdown::wrap_text(&e.to_string(), width, theme) {
                        let text: String = line.spans.iter().map(|s| s.content.as_ref()).collect();
                        lines.push(Line::from(Span::styled(
                            format!("       {text}"),
                            theme.dim(),
                        )));
                    }
                }
            }
            lines.push(Line::from(""));
            lines
        })
        .collect();
    if entries.is_empty() {
        Paragraph::new(Line::from(Span::styled(
            "   No lessons found. `--lessons DIR` loads the *.md files of DIR.",
            theme.fg(Color::Yellow),
        )))
        .render(list, buf);
    } else {
        // Scroll so that the selected entry is on screen.
        let height = usize::from(list.height);
        let selected = app.selected().min(entries.len() - 1);
        let mut first = 0;
        while first < selected
            && entries[first..=selected]
                .iter()
                .map(Vec::len)
                .sum::<usize>()
                > height
        {
            first += 1;
        }
        let lines: Vec<Line> = entries.into_iter().skip(first).flatten().collect();
        Paragraph::new(lines).render(list, buf);
    }
    Paragraph::new(message_lines).render(message, buf);
    buf.set_line(
        hints.x,
        hints.y,
        // The digits that open a lesson: as many as there are lessons, 9 at most.
        &Line::from(Span::styled(
            match app.lessons().len().min(9) {
                0 => " ? help · q quit".to_string(),
                1 => " ↑/↓ choose · Enter open · 1 lesson 1 · ? help · q quit".to_string(),
                n => format!(" ↑/↓ choose · Enter open · 1–{n} lesson N · ? help · q quit"),
            },
            theme.dim(),
        )),
        hints.width,
    );
}
