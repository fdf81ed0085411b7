//! Snapshots of the lesson app drawn into ratatui's `TestBackend` at 100 × 32: the menu, the
//! first step of every lesson (initial state: nothing depends on the wall clock), the help
//! overlay, a diverged run and the "terminal too small" message.
//!
//! After an intended change of the screens, review with `cargo insta review` (or accept with
//! `INSTA_UPDATE=always cargo test --test tui_snapshots`) and commit `tests/snapshots/`.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use springlab::lesson;
use springlab::tui::{App, Theme};

fn draw(app: &App, width: u16, height: u16) -> String {
    let mut terminal = Terminal::new(TestBackend::new(width, height)).expect("test backend");
    terminal
        .draw(|frame| frame.render_widget(app, frame.area()))
        .expect("draw");
    terminal.backend().to_string()
}

fn app() -> App {
    App::new(lesson::builtin(), Theme { color: false })
}

fn key(app: &mut App, code: KeyCode) {
    app.handle_key(KeyEvent::new(code, KeyModifiers::NONE));
}

#[test]
fn menu() {
    insta::assert_snapshot!("menu", draw(&app(), 100, 32));
}

#[test]
fn first_step_of_every_lesson() {
    let mut app = app();
    let lessons = app.lessons().to_vec();
    for (i, l) in lessons.iter().enumerate() {
        let l = l.as_ref().expect("built-in lessons load");
        app.open_lesson(i).expect("opens");
        insta::assert_snapshot!(format!("lesson_{}_step_1", l.number), draw(&app, 100, 32));
    }
}

#[test]
fn help_overlay() {
    let mut app = app();
    app.open_lesson(0).expect("opens");
    key(&mut app, KeyCode::Char('?'));
    insta::assert_snapshot!("help", draw(&app, 100, 32));
}

#[test]
fn diverged_run_shows_where_it_stopped() {
    let mut app = app();
    let euler = app.find_lesson("euler").expect("lesson 3");
    app.open_lesson(euler).expect("opens");
    // Explicit Euler on the rope (step 3) blows up within seconds.
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char('n'));
    key(&mut app, KeyCode::Char(' '));
    for _ in 0..100 {
        app.tick(0.1);
    }
    let run = app.lesson().expect("open");
    assert!(run.sim().diverged.is_some());
    assert!(!run.is_running());
    insta::assert_snapshot!("diverged", draw(&app, 100, 32));
}

#[test]
fn small_terminal_gets_a_message() {
    let mut app = app();
    app.open_lesson(0).expect("opens");
    insta::assert_snapshot!("too_small", draw(&app, 70, 20));
}

#[test]
fn smallest_supported_terminal() {
    let mut app = app();
    app.open_lesson(1).expect("opens");
    insta::assert_snapshot!("lesson_2_step_1_80x24", draw(&app, 80, 24));
}
