//! Every step fits the README's smallest terminal, 80 × 24: the try list (every item's keys)
//! and the goal are in the text column, before and after a prediction's answer, and the status lines
//! hold whole fields only (each field of the 80-column line is a field of the same line drawn
//! 240 columns wide: none is cut in the middle of a number). Every step's screen is kept in a
//! snapshot, one file per lesson, to look at.

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
        .map(|l| {
            // Each row is quoted: one quote off each end (a row's own quotes stay).
            let l = l.strip_prefix('"').unwrap_or(l);
            l.strip_suffix('"').unwrap_or(l).to_string()
        })
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
    // At least three rows of the step's text above the rule of the sections below it.
    if let Some(rule) = left.iter().position(|r| r.starts_with("────")) {
        assert!(
            rule >= 4,
            "{at}: {} rows of text\n{}",
            rule - 1,
            small.join("\n")
        );
    }
    // Before a prediction's answer nothing runs, and a try list that would leave no room for
    // the text waits as one line.
    let waiting = run.awaiting_prediction()
        && text.contains(&format!(
            "Try ({} items, after your prediction)",
            step.try_list.len()
        ));
    if !step.try_list.is_empty() {
        assert!(
            text.contains("Try"),
            "{at}: no try list\n{}",
            small.join("\n")
        );
        for (i, item) in step.try_list.iter().enumerate().filter(|_| !waiting) {
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
    // The scene pane's border titles (its top and bottom rows, the first of the right column
    // to hold a corner) hold whole fields only, as the status line does.
    let titles = |rows: &[String], from: usize| -> Vec<String> {
        let mut found = Vec::new();
        let right: Vec<String> = rows
            .iter()
            .map(|r| r.chars().skip(from).collect())
            .collect();
        let Some((t, column)) = right
            .iter()
            .enumerate()
            .find_map(|(i, r)| r.chars().position(|c| c == '┌').map(|c| (i, c)))
        else {
            return found;
        };
        let bottom = right[t..]
            .iter()
            .find(|r| r.chars().nth(column) == Some('└'));
        for r in std::iter::once(&right[t]).chain(bottom) {
            for segment in r.split(['┌', '└', '┐', '┘']) {
                let t = segment.trim_matches(|c: char| c == '─' || c == ' ' || c == '│');
                if !t.is_empty() && !t.starts_with('│') {
                    found.extend(fields(t));
                }
            }
        }
        found
    };
    let whole = titles(&wide, 0);
    for f in titles(&small, 40) {
        assert!(
            whole.contains(&f),
            "{at}: pane title \"{f}\" is cut (whole: {whole:?})\n{}",
            small.join("\n")
        );
    }
    // A status field the step points at (a try item, or a line of its text that says "status
    // line", names it) is on the 80-column line wherever the wide one has it.
    let named = |tag: &str| springlab::tui::status::points_at(run, tag);
    for (tag, field) in [
        ("dt·ω", "dt·ω "),
        ("stable below", "stable below "),
        ("`c`", "c "),
        ("γ", "γ "),
        ("`k`", "k "),
        ("k_d", "k_d "),
    ] {
        let has = |row: &str| fields(row).iter().any(|f| f.starts_with(field));
        if named(tag) && has(&wide[21]) {
            assert!(
                has(&small[21]),
                "{at}: the text names {tag}, the status line at 80 columns leaves it out: {}",
                small[21]
            );
        }
    }
    // A method's short label ("SIE") stands for its name where room is short.
    let short = |f: &str, all: &[String]| {
        let name = |label: &str| {
            springlab::physics::Method::ALL
                .iter()
                .find(|m| m.declaration().label == label)
                .map(|m| m.declaration().name)
        };
        let names: Option<Vec<&str>> = f.split(',').map(name).collect();
        names.is_some_and(|n| all.contains(&n.join(",")))
    };
    for row in [21, 22] {
        let all = fields(&wide[row]);
        for f in fields(&small[row]) {
            assert!(
                all.contains(&f) || short(&f, &all),
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

/// Every step of every lesson as a student meets it at 80 × 24 (and a prediction step again
/// after its answer) is checked, and kept in one snapshot per lesson to look at.
#[test]
fn every_step_fits_80x24_with_its_try_list_goal_and_whole_status_fields() {
    let mut app = app();
    let mut screens = 0;
    for (li, l) in lessons().iter().enumerate() {
        app.open_lesson(li).expect("opens");
        let mut lesson_screens = Vec::new();
        for si in 0..l.steps.len() {
            if si > 0 {
                key(&mut app, 'n');
            }
            let at = format!("lesson {} step {}", l.number, si + 1);
            check(&app, &at);
            lesson_screens.push(format!("── {at} ──\n{}", draw(&app, 80, 24).join("\n")));
            if app.lesson().expect("open").awaiting_prediction() {
                key(&mut app, '1');
                let at = format!("{at} after the answer");
                check(&app, &at);
                lesson_screens.push(format!("── {at} ──\n{}", draw(&app, 80, 24).join("\n")));
            }
        }
        screens += l.steps.len();
        insta::assert_snapshot!(
            format!("lesson_{}_80x24", l.number),
            lesson_screens.join("\n")
        );
    }
    // Every `+++ step` of the lesson files, none left out.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("lessons");
    let mut marked = 0;
    for entry in std::fs::read_dir(dir).expect("lessons/") {
        let text = std::fs::read_to_string(entry.expect("entry").path()).expect("a lesson file");
        marked += text.lines().filter(|l| l.trim_end() == "+++ step").count();
    }
    assert_eq!(screens, marked);
    assert!(screens >= 34, "{screens} steps");
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

/// The menu at 80 × 24: a lesson's line shows the command that opens it whole or not at all
/// (cut at the edge it would be a command that does not work); at 120 columns every lesson
/// shows it. Scrolled down, every lesson's line is checked.
#[test]
fn menu_commands_are_whole_or_left_out() {
    let mut app = app();
    let count = app.lessons().len();
    let mut seen = std::collections::BTreeSet::new();
    for i in 0..count {
        for row in draw(&app, 80, 24) {
            let ticks = row.matches('`').count();
            assert!(ticks % 2 == 0, "a command cut at the edge: {row:?}");
            if let Some(at) = row.find("`springlab lesson ") {
                let command = row[at + 1..]
                    .split('`')
                    .next()
                    .unwrap_or_default()
                    .to_owned();
                seen.insert(command);
            }
        }
        if i + 1 < count {
            app.handle_key(KeyEvent::new(KeyCode::Down, KeyModifiers::NONE));
        }
    }
    assert!(!seen.is_empty(), "no command shown at 80 columns");
    let wide = draw(&app, 120, 60).join("\n");
    for l in lessons() {
        let command = format!("`springlab lesson {}`", l.slug);
        assert!(wide.contains(&command), "{command} missing at 120 columns");
    }
}
