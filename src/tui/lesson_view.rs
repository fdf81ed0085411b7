//! The lesson screen: the step's title, its text on the left with the "try" list and the goal
//! below it, the scene and the step's plots on the right, and two status lines at the bottom.
//! It reads the run ([`LessonRun`]) and changes nothing.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use super::plots::{self};
use super::sim_view::{self, Painter};
use super::{Theme, markdown, status};
use crate::lesson::Plot;
use crate::physics::Method;

use super::lesson_run::{Chooser, LessonRun, method_key};

/// Draws the lesson screen; returns the scene canvas's inner area (for the mouse).
pub fn render(
    run: &LessonRun,
    fps: Option<f64>,
    view: &str,
    theme: Theme,
    painter: &dyn Painter,
    area: Rect,
    buf: &mut Buffer,
) -> Rect {
    let [header, body, status_area, hints] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Fill(1),
        Constraint::Length(2),
        Constraint::Length(1),
    ])
    .areas(area);
    render_header(run, theme, header, buf);
    let [left, right] = columns(body);
    render_text(run, theme, left, buf);
    let shown = shown_plots(run, right);
    let (scene, plot_area) = split_right(&shown, right);
    let canvas = sim_view::render(run, theme, painter, scene, buf);
    if let Some(plot_area) = plot_area {
        render_plots(run, &shown, theme, plot_area, buf);
        // Where only one of the step's plots fits, its bottom border says how to see the others.
        let all = run.shown_plots().len();
        if shown.len() < all {
            let hint = format!(" Tab: plot {} of {all} ", run.plot_turn() % all + 1);
            let w = hint.chars().count() as u16;
            if plot_area.width > w + 2 && plot_area.height > 0 {
                buf.set_string(
                    plot_area.x + plot_area.width - w - 1,
                    plot_area.y + plot_area.height - 1,
                    hint,
                    theme.fg(Color::Yellow),
                );
            }
        }
    }
    status::render(run, fps, view, theme, status_area, buf);
    render_hints(run, theme, hints, buf);
    canvas
}

/// The step's plots side by side: lesson 8's from the run's readings and the recorded studies
/// (`observed_view`), the others by `plots`.
fn render_plots(run: &LessonRun, shown: &[Plot], theme: Theme, area: Rect, buf: &mut Buffer) {
    let own = |p: &Plot| matches!(p, Plot::Observable | Plot::Resolution);
    let (mine, others): (Vec<Plot>, Vec<Plot>) = shown.iter().partition(|p| own(p));
    let count = shown.len().max(1) as u16;
    let width = area.width / count;
    let others_width = if mine.is_empty() {
        area.width
    } else {
        width * others.len() as u16
    };
    if !others.is_empty() {
        plots::render(
            &others,
            run.history(),
            run.oscillator(),
            run.studies(),
            run.shown_methods(),
            run.sim().time(),
            theme,
            Rect::new(area.x, area.y, others_width, area.height),
            buf,
        );
    }
    for (i, plot) in mine.iter().enumerate() {
        let x = area.x + others_width + width * i as u16;
        let w = if i + 1 == mine.len() {
            area.x + area.width - x
        } else {
            width
        };
        super::observed_view::render(*plot, run, theme, Rect::new(x, area.y, w, area.height), buf);
    }
}

/// Narrowest a plot is drawn (columns): below it the step's plots collapse to the first.
pub const MIN_PLOT_WIDTH: u16 = 28;

/// The text column and the right column of the body: 40 % for the text, 50 % on terminals
/// under 100 columns (where the try list and goal would wrap too much).
fn columns(body: Rect) -> [Rect; 2] {
    let text = if body.width < 100 { 50 } else { 40 };
    Layout::horizontal([Constraint::Percentage(text), Constraint::Fill(1)]).areas(body)
}

/// The plots shown now (see [`LessonRun::shown_plots`]), only one when the right column is too
/// narrow for them side by side: the one Tab turned to ([`LessonRun::plot_turn`]).
fn shown_plots(run: &LessonRun, right: Rect) -> Vec<Plot> {
    let plots = run.shown_plots();
    if plots.len() > 1 && right.width / (plots.len() as u16) < MIN_PLOT_WIDTH {
        return vec![plots[run.plot_turn() % plots.len()]];
    }
    plots
}

/// The scene pane and the plots' area of the right column (no plots: the whole column).
fn split_right(plots: &[Plot], right: Rect) -> (Rect, Option<Rect>) {
    if plots.is_empty() {
        return (right, None);
    }
    // Study charts (log-log, several methods) get more of the column than time plots.
    let share = if plots.iter().any(|p| p.is_study()) {
        3
    } else {
        2
    };
    let plot_height = (right.height * share / 5)
        .max(8)
        .min(right.height.saturating_sub(6));
    let [scene, plot_area] =
        Layout::vertical([Constraint::Fill(1), Constraint::Length(plot_height)]).areas(right);
    (scene, Some(plot_area))
}

/// The scene pane's inner area (inside its border) when the lesson screen fills `area`.
#[must_use]
pub fn scene_inner(run: &LessonRun, area: Rect) -> Rect {
    let [_, body, _, _] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Fill(1),
        Constraint::Length(2),
        Constraint::Length(1),
    ])
    .areas(area);
    let [_, right] = columns(body);
    let (scene, _) = split_right(&shown_plots(run, right), right);
    ratatui::widgets::Block::bordered().inner(scene)
}

/// The plots shown and the plots' area when the lesson screen fills `area` (`None` without
/// plots).
#[must_use]
pub fn plots_area(run: &LessonRun, area: Rect) -> Option<(Vec<Plot>, Rect)> {
    let [_, body, _, _] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Fill(1),
        Constraint::Length(2),
        Constraint::Length(1),
    ])
    .areas(area);
    let [_, right] = columns(body);
    let shown = shown_plots(run, right);
    let (_, plot_area) = split_right(&shown, right);
    plot_area.map(|a| (shown, a))
}

fn render_header(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let lesson = run.lesson();
    let bold = Style::new().add_modifier(Modifier::BOLD);
    let name = format!(" Lesson {}: {}", lesson.number, lesson.title);
    let step = format!("step {}/{}: ", run.step_index() + 1, lesson.steps.len());
    // The step's title ends in "…" where it is cut (the lesson's name gives way first).
    let room = usize::from(area.width).saturating_sub(step.chars().count() + 2);
    let title = ellipsis(run.shown_title(), room);
    let name = ellipsis(
        &name,
        usize::from(area.width).saturating_sub(step.chars().count() + title.chars().count() + 3),
    ) + " ";
    let line = Line::from(vec![
        Span::styled(name, bold.patch(theme.fg(Color::Cyan))),
        Span::styled("· ", theme.dim()),
        Span::styled(format!("{step}{title}"), bold),
    ]);
    buf.set_line(area.x, area.y, &line, area.width);
    let right = "? help · q menu ";
    let width = right.chars().count() as u16;
    if area.width > width + line.width() as u16 + 2 {
        buf.set_string(area.x + area.width - width, area.y, right, theme.dim());
    }
}

/// The step text (scrollable with PgUp / PgDn; code sideways with h / l) above the "try"
/// list, the prediction and the goal.
fn render_text(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let area = Rect {
        width: area.width.saturating_sub(1),
        ..area
    };
    let width = area.width.saturating_sub(1).max(10);
    let step = run.step();
    let bold_green = Style::new()
        .add_modifier(Modifier::BOLD)
        .patch(theme.fg(Color::Green));
    let key_style = theme.fg(Color::Cyan).add_modifier(Modifier::BOLD);
    // The prediction (its heading, then the question and options), the try list and the goal,
    // each a section below the text. When they do not fit with a few rows of text: once the
    // answer is out, the question and options give way (the reveal names the answer), then
    // the explanation and the reveal move to the top of the scrolling text (never dropped);
    // the try list and the goal always show.
    let mut head: Vec<Line<'static>> = Vec::new();
    let mut tail: Vec<Line<'static>> = Vec::new();
    let mut reveal: Vec<Line<'static>> = Vec::new();
    let mut explain: Vec<Line<'static>> = Vec::new();
    if let Some(p) = &step.predict {
        head.push(Line::from(vec![
            Span::styled("Predict ", bold_green),
            Span::styled(
                match run.answer() {
                    None => format!("1–{} first", p.options.len()),
                    Some(a) => format!("you chose {}", a + 1),
                },
                theme.fg(Color::Yellow),
            ),
        ]));
        tail.extend(markdown::wrap_text(&p.question, width, theme));
        for (i, o) in p.options.iter().enumerate() {
            let mark = match (run.answer(), run.revealed()) {
                (_, Some(_)) if i == p.answer => "✓",
                (Some(a), _) if a == i => "▸",
                _ => " ",
            };
            let mut lines =
                markdown::wrap_text(&format!("{}) {}", i + 1, o.text), width - 2, theme);
            for (j, l) in lines.iter_mut().enumerate() {
                let mut spans = vec![Span::styled(
                    if j == 0 {
                        format!("{mark} ")
                    } else {
                        "  ".into()
                    },
                    key_style,
                )];
                spans.append(&mut l.spans);
                *l = Line::from(spans);
            }
            tail.extend(lines);
        }
        if let Some(r) = run.revealed() {
            reveal = markdown::wrap_text(r, width, theme)
                .into_iter()
                .map(|l| l.patch_style(theme.fg(Color::LightGreen)))
                .collect();
            if !p.explain.is_empty() {
                explain = markdown::wrap_text(&p.explain, width, theme);
            }
        }
    }
    let mut rest: Vec<Line<'static>> = Vec::new();
    if !step.try_list.is_empty() {
        let restart = step.try_list.iter().any(|t| {
            t.keys
                .as_ref()
                .is_some_and(crate::lesson::Keys::from_step_start)
        });
        rest.push(Line::from(vec![
            Span::styled("Try", bold_green),
            Span::styled(
                if restart {
                    "  (R: from the step's start)"
                } else {
                    ""
                },
                theme.dim(),
            ),
        ]));
        for (i, item) in step.try_list.iter().enumerate() {
            if !run.try_shown(i) {
                rest.push(Line::styled(
                    "• (after your prediction)".to_string(),
                    theme.dim(),
                ));
                continue;
            }
            let mut lines = markdown::bullet(&item.text, width, theme);
            if let Some(keys) = &item.keys {
                let k = format!("  keys: {keys}");
                let fits = lines
                    .last()
                    .is_some_and(|l| l.width() + k.chars().count() <= usize::from(width));
                if fits {
                    if let Some(l) = lines.last_mut() {
                        l.spans.push(Span::styled(k, key_style));
                    }
                } else {
                    lines.push(Line::from(Span::styled(
                        format!("  keys: {keys}"),
                        key_style,
                    )));
                }
            }
            rest.extend(lines);
        }
    }
    let try_rows = rest.len();
    if let Some(goal) = &step.goal {
        let (mark, style) = match run.goal_state() {
            Some(true) => ("✓ met", theme.fg(Color::LightGreen)),
            Some(false) => ("✗ failed: r to retry", theme.fg(Color::LightRed)),
            None => ("… pending", theme.fg(Color::Yellow)),
        };
        rest.push(Line::from(vec![
            Span::styled("Goal ", bold_green),
            Span::styled(mark, style.add_modifier(Modifier::BOLD)),
        ]));
        if run.goal_shown() {
            rest.extend(markdown::wrap_text(&goal.text, width, theme));
        } else {
            rest.push(Line::styled(
                "(after your prediction)".to_string(),
                theme.dim(),
            ));
        }
    }
    // At least four rows of text (three and its scroll hint) above the rule.
    let room = usize::from(area.height.saturating_sub(5));
    let over = |parts: &[&Vec<Line<'static>>]| parts.iter().map(|p| p.len()).sum::<usize>() > room;
    if !reveal.is_empty() && over(&[&head, &tail, &reveal, &explain, &rest]) {
        tail.clear();
    } else if let (Some(p), Some(a)) = (&step.predict, run.answer())
        && over(&[&head, &tail, &rest])
    {
        // Answered, the run to come: the chosen option stands for the question and the others.
        tail = markdown::wrap_hanging(
            &format!("{}) {}", a + 1, p.options[a].text),
            width,
            "▸ ",
            "  ",
            theme,
        );
    }
    // Before the answer nothing runs: a try list that leaves no room for the text waits for
    // the answer as one line.
    if run.awaiting_prediction() && try_rows > 1 && over(&[&head, &tail, &rest]) {
        rest.splice(
            0..try_rows,
            [Line::from(vec![
                Span::styled("Try", bold_green),
                Span::styled(
                    format!("  ({} items, after your prediction)", step.try_list.len()),
                    theme.dim(),
                ),
            ])],
        );
    }
    // Lines that open the scrolling text instead of the section below it.
    let mut opening: Vec<Line<'static>> = Vec::new();
    if over(&[&head, &tail, &reveal, &explain, &rest]) {
        opening = std::mem::take(&mut explain);
        if over(&[&head, &tail, &reveal, &rest]) {
            opening.splice(0..0, std::mem::take(&mut reveal));
        }
        if !opening.is_empty() {
            opening.push(Line::default());
        }
    }
    let tail: Vec<Line<'static>> = head
        .into_iter()
        .chain(tail)
        .chain(reveal)
        .chain(explain)
        .chain(rest)
        .collect();
    let tail_height = (tail.len() as u16).min(area.height.saturating_sub(1));
    let [text_area, tail_area] = Layout::vertical([
        Constraint::Fill(1),
        Constraint::Length(if tail.is_empty() { 0 } else { tail_height + 1 }),
    ])
    .areas(area);
    // Plain text: the Markdown subset shown here has no italics (`*…*` would show its stars).
    let shown = if run.text_held_back() {
        run.shown_text().trim_end()
    } else {
        run.shown_text()
    };
    let held = match (run.text_held_back(), shown.is_empty()) {
        (false, _) => "",
        (true, true) => "(The rest of this step's text follows your prediction.)",
        (true, false) => "\n\n(The rest of this step's text follows your prediction.)",
    };
    let marked: Vec<(Line<'static>, bool)> = opening
        .into_iter()
        .map(|l| (l, false))
        .chain(markdown::render_marked(
            &format!("{shown}{held}"),
            width,
            theme,
        ))
        .collect();
    let total = marked.len() as u16;
    // When the text does not fit, its last row holds the scroll hint (never over the text).
    let overflow = total > text_area.height;
    let rows = if overflow {
        text_area.height.saturating_sub(1)
    } else {
        text_area.height
    };
    let max_scroll = total.saturating_sub(rows);
    run.set_text_rows(rows);
    let scroll = run.text_scroll().min(max_scroll);
    let marker = theme.fg(Color::Yellow).add_modifier(Modifier::BOLD);
    let offset = usize::from(run.hscroll());
    let shown: Vec<Line<'static>> = marked
        .into_iter()
        .skip(usize::from(scroll))
        .take(usize::from(rows))
        .map(|(line, code)| {
            if code {
                markdown::clip(&line, offset, usize::from(text_area.width), marker)
            } else {
                line
            }
        })
        .collect();
    Paragraph::new(shown).render(
        Rect {
            height: rows,
            ..text_area
        },
        buf,
    );
    if overflow && text_area.height > 0 {
        let hint = match (scroll > 0, scroll < max_scroll) {
            (false, _) => " ↓ more: PgDn ",
            (true, true) => " ↑ PgUp · ↓ PgDn ",
            (true, false) => " ↑ PgUp: back ",
        };
        let w = hint.chars().count() as u16;
        buf.set_string(
            text_area.x + text_area.width.saturating_sub(w),
            text_area.y + text_area.height - 1,
            hint,
            theme.fg(Color::Yellow).add_modifier(Modifier::REVERSED),
        );
    }
    if !tail.is_empty() && tail_area.height > 0 {
        let rule = "─".repeat(tail_area.width as usize);
        buf.set_string(tail_area.x, tail_area.y, rule, theme.dim());
        let rest = Rect {
            y: tail_area.y + 1,
            height: tail_area.height - 1,
            ..tail_area
        };
        Paragraph::new(tail).render(rest, buf);
    }
    if let Some(c) = run.chooser() {
        render_chooser(run, c, theme, area, buf);
    }
}

/// The method chooser over the bottom of the text column.
fn render_chooser(run: &LessonRun, c: &Chooser, theme: Theme, area: Rect, buf: &mut Buffer) {
    let bodies = &run.sim().scene.bodies;
    let current = |m: Method| match c.target {
        Some(b) => bodies.get(b).is_some_and(|b| b.method == m),
        None => bodies.iter().all(|b| b.method == m),
    };
    let mut lines: Vec<Line> = Method::ALL
        .iter()
        .enumerate()
        .map(|(i, &m)| {
            let style = if i == c.selected {
                Style::new().add_modifier(Modifier::REVERSED)
            } else {
                Style::new()
            };
            Line::from(vec![
                Span::styled(
                    format!(" {} {} ", i + 1, method_key(m)),
                    theme.fg(Color::Cyan).add_modifier(Modifier::BOLD),
                ),
                Span::styled(
                    format!("{}{}", m.name(), if current(m) { " (now)" } else { "" }),
                    style,
                ),
            ])
        })
        .collect();
    if bodies.len() > 1 {
        let target = c
            .target
            .and_then(|b| bodies.get(b))
            .map_or("every body".to_string(), |b| b.label.clone());
        lines.push(Line::styled(
            format!(" Tab: for {target}"),
            theme.fg(Color::Yellow),
        ));
    }
    lines.push(Line::styled(" key, number or Enter · Esc", theme.dim()));
    let height = (lines.len() as u16 + 2).min(area.height);
    let width = 36.min(area.width);
    let rect = Rect::new(area.x, area.y + area.height - height, width, height);
    ratatui::widgets::Clear.render(rect, buf);
    Paragraph::new(lines)
        .block(
            ratatui::widgets::Block::bordered()
                .title(" method (m) ")
                .border_style(theme.fg(Color::Cyan)),
        )
        .render(rect, buf);
}

/// `text` cut to `room` characters, its last one "…" where it is cut.
fn ellipsis(text: &str, room: usize) -> String {
    if text.chars().count() <= room {
        return text.to_string();
    }
    // The file format's excerpt, without a space before its "…".
    let cut = crate::scene::file::excerpt(text, room.saturating_sub(1));
    format!("{}…", cut.trim_end_matches('…').trim_end())
}

fn render_hints(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let line = match run.message() {
        Some(m) => Line::from(Span::styled(
            ellipsis(&format!(" {m}"), usize::from(area.width)),
            theme.fg(Color::Yellow),
        )),
        None => {
            // The longest hint that fits, so that "? help · q menu" is never cut off.
            let hints = [
                " space run · s step · r reset · m method · +/- dt · k/K d/D a/A · v view · \
                 n/p step · ? help · q menu",
                " space run · s step · r reset · m method · +/- dt · v view · n/p step · ? help \
                 · q menu",
                " space run · r reset · m method · +/- dt · n/p step · ? help · q menu",
                " space run · ? help · q menu",
            ];
            let fits = hints
                .iter()
                .find(|h| h.chars().count() <= usize::from(area.width))
                .unwrap_or(&hints[hints.len() - 1]);
            Line::from(Span::styled(*fits, theme.dim()))
        }
    };
    buf.set_line(area.x, area.y, &line, area.width);
}
