//! No prediction is spoiled: before the student answers, the screen of a step with a prediction
//! (drawn at 120 × 40 and at 80 × 24) shows none of what its front matter keeps back (the step's
//! own title, the hidden try items, the text from `from` on, the goal's text, the hidden plots'
//! titles, the status line's limit) nor the words that give each built-in prediction's answer
//! away, and the step before shows none of its hidden plots; after the answer the step's title
//! and every try item are there.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::lesson::{self, Lesson};
use springlab::tui::{App, ColourDepth, Graphics, Theme, ViewMode};

/// The screen's text: its rows joined, then the text column's rows joined (the left 40 % or,
/// under 100 columns, half), so that a phrase wrapped over two rows of the column is found.
fn draw(app: &App, width: u16, height: u16) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(app, frame.area()))
        .expect("draw");
    let rows: Vec<String> = terminal
        .backend()
        .to_string()
        .lines()
        .map(|l| {
            // Each row is quoted: one quote off each end (a row's own quotes stay).
            let l = l.strip_prefix('"').unwrap_or(l);
            l.strip_suffix('"').unwrap_or(l).to_string()
        })
        .collect();
    let column = usize::from(if width < 100 {
        width / 2
    } else {
        width * 2 / 5
    });
    let left: Vec<String> = rows
        .iter()
        .map(|r| r.chars().take(column).collect())
        .collect();
    format!("{} | {}", rows.join(" "), left.join(" "))
}

/// Collapses runs of spaces (the screen pads, the text wraps).
fn squeeze(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Words that answer each built-in prediction: (lesson, step, phrases).
const ANSWERS: &[(u32, usize, &[&str])] = &[
    (
        3,
        2,
        &[
            "Semi-implicit Euler keeps",
            "does not grow",
            "blow up too",
            "symplectic",
        ],
    ),
    (
        5,
        6,
        &[
            "fails first",
            "explodes at the impact",
            "it survives",
            "half of",
        ],
    ),
    (7, 2, &["2√2", "2.83", "dt·ω ≤ 1", "stable dt·ω"]),
];

fn lessons() -> Vec<Lesson> {
    lesson::builtin()
        .into_iter()
        .map(|l| l.expect("built-in lessons load"))
        .collect()
}

#[test]
fn no_prediction_step_shows_its_answer_before_it_is_given() {
    let mut checked = Vec::new();
    for (li, l) in lessons().iter().enumerate() {
        for (si, step) in l.steps.iter().enumerate() {
            let Some(p) = &step.predict else { continue };
            let mut app = App::new(lesson::builtin(), Theme::PLAIN).with_display(
                ViewMode::Braille,
                Graphics::NONE,
                ColourDepth::None,
            );
            app.open_lesson(li).expect("opens");
            for _ in 0..si {
                app.handle_key(KeyEvent::new(KeyCode::Char('n'), KeyModifiers::NONE));
            }
            let run = app.lesson().expect("open");
            assert!(run.awaiting_prediction());
            let mut secrets: Vec<String> = Vec::new();
            let hide = &step.hide;
            if hide.title.is_some() {
                secrets.push(step.title.clone());
            }
            for &i in &hide.try_items {
                secrets.push(step.try_list[i].text.clone());
            }
            if hide.goal {
                secrets.extend(step.goal.iter().map(|g| g.text.clone()));
            }
            let full = run.text().to_string();
            if hide.from.is_some() {
                // Each hidden line's first words (a line of Markdown fits any column).
                for line in full[hide.text_before(&full).len()..].lines() {
                    let words: Vec<&str> = line.split_whitespace().take(4).collect();
                    if words.len() == 4 {
                        secrets.push(words.join(" "));
                    }
                }
            }
            secrets.push(p.explain.clone());
            if let Some((_, _, words)) = ANSWERS
                .iter()
                .find(|(n, s, _)| *n == l.number && *s == si + 1)
            {
                secrets.extend(words.iter().map(|w| (*w).to_string()));
                checked.push((l.number, si + 1));
            }
            // A prediction about blowing up or surviving keeps the limit back: dt against the
            // limit on the status line answers it.
            let stability = p.options.iter().any(|o| {
                matches!(
                    o.claim.kind,
                    lesson::GoalKind::Survive | lesson::GoalKind::Diverge
                )
            });
            assert!(
                !stability || hide.limit,
                "lesson {} step {}: a stability prediction that shows the limit (hide.limit)",
                l.number,
                si + 1
            );
            // A plot kept back here is not on the step before either (the student has just
            // seen it there).
            if si > 0 {
                for plot in &hide.plots {
                    assert!(
                        !l.steps[si - 1].plots.contains(plot),
                        "lesson {} step {} shows the {plot:?} plot that step {} keeps back",
                        l.number,
                        si,
                        si + 1
                    );
                }
            }
            for (w, h) in [(120, 40), (80, 24)] {
                let screen = squeeze(&draw(&app, w, h));
                if hide.limit {
                    let numbered = |field: &str| {
                        screen.match_indices(field).any(|(i, _)| {
                            screen[i + field.len()..]
                                .chars()
                                .next()
                                .is_some_and(|c| c.is_ascii_digit())
                        })
                    };
                    for field in ["limit ", "stable below ", "dt·ω "] {
                        assert!(
                            !numbered(field),
                            "lesson {} step {} at {w}×{h} shows \"{field}…\" before the answer:\n{screen}",
                            l.number,
                            si + 1
                        );
                    }
                    assert!(screen.contains("limit: after your prediction"), "{screen}");
                }
                for secret in &secrets {
                    assert!(
                        !screen.contains(&squeeze(secret)),
                        "lesson {} step {} at {w}×{h} shows \"{secret}\" before the answer:\n{screen}",
                        l.number,
                        si + 1
                    );
                }
            }
            app.handle_key(KeyEvent::new(KeyCode::Char('1'), KeyModifiers::NONE));
            let screen = squeeze(&draw(&app, 120, 40));
            let title = squeeze(&step.title);
            assert!(
                screen.contains(&title),
                "lesson {} step {}: the title after the answer",
                l.number,
                si + 1
            );
            let run = app.lesson().expect("open");
            assert!((0..step.try_list.len()).all(|i| run.try_shown(i)));
            assert_eq!(run.shown_text(), run.text());
        }
    }
    for (n, s, _) in ANSWERS {
        assert!(
            checked.contains(&(*n, *s)),
            "lesson {n} step {s} has a prediction"
        );
    }
}
