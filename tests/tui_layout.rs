//! Every step fits the README's smallest terminal, 80 × 24: the try list (every item's keys)
//! and the goal are in the text column, before and after a prediction's answer, and the status lines
//! hold whole fields only (each field of the 80-column line is a field of the same line drawn
//! 240 columns wide: none is cut in the middle of a number). Two prediction steps are kept as
//! snapshots to look at.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::lesson::{self, Lesson};
use springlab::tui::status::precise;
use springlab::tui::{App, ColourDepth, Graphics, Theme, ViewMode};

fn draw(app: &App, width: u16, height: u16) -> Vec<String> {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(app, frame.area()))
        .expect("draw");
    terminal
        .backend()
        .to_string()
        .lines()
        .map(|l| l.trim_matches('"').to_string())
        .collect()
}

fn squeeze(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn app() -> App {
    App::new(lesson::builtin(), Theme::PLAIN).with_display(
        ViewMode::Braille,
        Graphics::NONE,
        ColourDepth::None,
    )
}

fn key(app: &mut App, c: char) {
    app.handle_key(KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE));
}

/// The fields of a status line (` · ` between them).
fn fields(line: &str) -> Vec<String> {
    line.split(" · ").map(|f| f.trim().to_string()).collect()
}

/// Checks the screen of `app` at 80 × 24 (`at` names it).
fn check(app: &App, at: &str) {
    let run = app.lesson().expect("open");
    let step = run.step();
    let small = draw(app, 80, 24);
    let wide = draw(app, 240, 24);
    // The text column: the left half of an 80-column screen.
    let left: Vec<String> = small.iter().map(|r| r.chars().take(40).collect()).collect();
    let text = squeeze(&left.join(" "));
    if !step.try_list.is_empty() {
        assert!(
            text.contains("Try"),
            "{at}: no try list\n{}",
            small.join("\n")
        );
        for (i, item) in step.try_list.iter().enumerate() {
            if let (Some(keys), true) = (&item.keys, run.try_shown(i)) {
                assert!(
                    text.contains(&format!("keys: {keys}")),
                    "{at}: try {} keys \"{keys}\" not on screen\n{}",
                    i + 1,
                    small.join("\n")
                );
            }
        }
    }
    if let Some(goal) = &step.goal {
        assert!(text.contains("Goal"), "{at}: no goal\n{}", small.join("\n"));
        if run.goal_shown() {
            assert!(
                text.contains(&squeeze(&goal.text)),
                "{at}: the goal's text is not whole on screen\n{}",
                small.join("\n")
            );
        }
    }
    for row in [21, 22] {
        let all = fields(&wide[row]);
        for f in fields(&small[row]) {
            assert!(
                all.contains(&f),
                "{at}: status field \"{f}\" is cut (whole: {all:?})"
            );
        }
    }
}

fn lessons() -> Vec<Lesson> {
    lesson::builtin()
        .into_iter()
        .map(|l| l.expect("built-in lessons load"))
        .collect()
}

#[test]
fn every_step_fits_80x24_with_its_try_list_goal_and_whole_status_fields() {
    let mut app = app();
    for (li, l) in lessons().iter().enumerate() {
        app.open_lesson(li).expect("opens");
        for si in 0..l.steps.len() {
            if si > 0 {
                key(&mut app, 'n');
            }
            let at = format!("lesson {} step {}", l.number, si + 1);
            check(&app, &at);
            if app.lesson().expect("open").awaiting_prediction() {
                key(&mut app, '1');
                check(&app, &format!("{at} after the answer"));
                if (l.number, si + 1) == (7, 2) || (l.number, si + 1) == (5, 6) {
                    insta::assert_snapshot!(
                        format!("lesson_{}_step_{}_80x24", l.number, si + 1),
                        draw(&app, 80, 24).join("\n")
                    );
                }
            }
        }
    }
}

/// dt and its limit print with enough digits to compare them.
#[test]
fn time_steps_print_four_significant_digits() {
    assert_eq!(precise(0.001_917_2), "1.917e-3");
    assert_eq!(precise(0.002), "2e-3");
    assert_eq!(precise(0.2), "0.2");
    assert_eq!(precise(0.282_842_7), "0.2828");
    assert_eq!(precise(8.49e-5), "8.49e-5");
    assert_eq!(precise(1e-4), "1e-4");
    assert_eq!(precise(0.01), "0.01");
}
